// Bad use gets a VciException that says what was wrong (or the exception the manual or .NET
// names), never a crash of the program or of canemud.
using System;
using System.Collections;
using System.Threading;
using Ixxat.Vci3;
using Ixxat.Vci3.Bal.Can;
using Ixxat.Vci3.Bal.Lin;
using NUnit.Framework;

namespace Canemu.Tests
{
  [TestFixture]
  public class BadUseTests
  {
    [Test]
    public void MessagesRefuseWhatTheyCannotHold()
    {
      var m = new CanMessage();
      var e = T.Throws(() => m.DataLength = 9);
      StringAssert.Contains("CanMessage.DataLength 9 is above 8", e.Message);
      Assert.Throws<IndexOutOfRangeException>(() => m[8] = 1);
      Assert.Throws<IndexOutOfRangeException>(() => { var b = m[-1]; });
      var l = new LinMessage();
      T.Throws(() => l.DataLength = 9);
      Assert.Throws<IndexOutOfRangeException>(() => l[8] = 1);
    }

    [Test]
    public void DisposedObjectsNullsAndWrongEventsSayWhat()
    {
      using (var daemon = new Daemon(Daemon.TwoAdapters))
      using (var alpha = new Line("alpha"))
      {
        var e = T.Throws(() => alpha.Writer.SendMessage(T.Msg(0x800, 1)));
        Assert.AreEqual(0xE0010004u, e.ErrorCode);
        StringAssert.Contains("identifier 0x800 does not fit 11 bits", e.Message);
        e = T.Throws(() => alpha.Writer.SendMessages(null));
        StringAssert.Contains("the array is null", e.Message);
        T.Throws(() => alpha.Reader.ReadMessages(null));
        e = T.Throws(() => alpha.Reader.AssignEvent((WaitHandle)null));
        StringAssert.Contains("the event is null", e.Message);
        e = T.Throws(() => alpha.Reader.AssignEvent(new Mutex()));
        StringAssert.Contains("Mutex cannot be signalled; pass an AutoResetEvent or a ManualResetEvent", e.Message);
        e = T.Throws(() => alpha.Control.InitLine(CanOperatingModes.Standard, CanBitrate.Empty));
        StringAssert.Contains("the bit rate is empty", e.Message);
        e = T.Throws(() => alpha.Control.DetectBaud(10, new CanBitrate[0]));
        StringAssert.Contains("the table must hold 1..64 bit rates", e.Message);
        using (var list = T.Open<ICanScheduler>(alpha.Bal))
        {
          e = T.Throws(() => list.AddMessage(null));
          StringAssert.Contains("the message is null", e.Message);
          e = T.Throws(() => new CanCyclicTXMsg().Start());
          StringAssert.Contains("the message is on no cyclic list", e.Message);
        }
        alpha.Channel.Dispose();
        alpha.Channel.Dispose();  // twice is fine
        e = T.Throws(() => alpha.Channel.Activate());
        Assert.AreEqual(0xE0010006u, e.ErrorCode);
        StringAssert.Contains("ICanChannel is disposed", e.Message);
        CanMessage unread;
        e = T.Throws(() => alpha.Reader.ReadMessage(out unread));
        StringAssert.Contains("ICanMessageReader is disposed", e.Message);
        alpha.Bal.Dispose();
        e = T.Throws(() => alpha.Bal.OpenSocket(0, typeof(ICanSocket)));
        StringAssert.Contains("IBalObject is disposed", e.Message);
        IEnumerator en = VciServer.GetDeviceManager().GetDeviceList().GetEnumerator();
        Assert.Throws<InvalidOperationException>(() => { var x = en.Current; });
        Assert.IsTrue(daemon.Running);
      }
    }

    [Test]
    public void WithoutCanemudEveryCallSaysWhereItLooked()
    {
      string socket;
      using (var daemon = new Daemon(Daemon.TwoAdapters))
      using (var alpha = new Line("alpha"))
      {
        socket = daemon.Socket;
        daemon.Dispose();  // canemud goes away under the open objects
        Thread.Sleep(200);
        var e = T.Throws(() => { for (int i = 0; i < 100; i++) { alpha.Writer.SendMessage(T.Msg(1)); Thread.Sleep(20); } });
        StringAssert.Contains("canemud", e.Message);
        e = T.Throws(() => alpha.Control.StopLine());
        StringAssert.Contains("ICanControl.StopLine: ", e.Message);
        StringAssert.Contains("canemud", e.Message);
      }
      var x = T.Throws(() => T.Devices());
      StringAssert.Contains("canemud is not running at " + socket, x.Message);
    }
  }
}
