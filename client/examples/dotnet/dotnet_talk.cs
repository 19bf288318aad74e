// A VCI .NET program that talks with whoever is on its adapter's bus (tests/python runs it with
// a python-can program on the same bus): it sends 100h 01 02 03, waits for 200h, answers with
// 101h and the bytes of 200h each + 1, and prints what it got. Real time; exits 1 when nothing
// comes within 10 s.
//
//   CANEMU_SOCKET=... MONO_PATH=build/lib mono build/bin/dotnet_talk.exe ADAPTER
using System;
using System.Collections;
using System.Threading;
using Ixxat.Vci3;
using Ixxat.Vci3.Bal;
using Ixxat.Vci3.Bal.Can;

static class DotnetTalk
{
  static int Main(string[] args)
  {
    string name = args.Length > 0 ? args[0] : "ixxat0";
    IVciDevice device = null;
    using (IVciDeviceManager manager = VciServer.GetDeviceManager())
    using (IVciDeviceList list = manager.GetDeviceList())
    {
      IEnumerator e = list.GetEnumerator();
      while (e.MoveNext())
      {
        var d = (IVciDevice)e.Current;
        if (d.Description.Contains("canemu " + name + ")")) device = d;
      }
    }
    if (device == null) { Console.Error.WriteLine("dotnet_talk: no adapter " + name); return 2; }

    using (IBalObject bal = device.OpenBusAccessLayer())
    using (var channel = (ICanChannel)bal.OpenSocket(0, typeof(ICanChannel)))
    using (var control = (ICanControl)bal.OpenSocket(0, typeof(ICanControl)))
    {
      channel.Initialize(64, 16, false);
      ICanMessageReader reader = channel.GetMessageReader();
      ICanMessageWriter writer = channel.GetMessageWriter();
      var received = new AutoResetEvent(false);
      reader.Threshold = 1;
      reader.AssignEvent(received);
      channel.Activate();
      control.InitLine(CanOperatingModes.Standard | CanOperatingModes.ErrFrame, CanBitrate.Cia500KBit);
      control.SetAccFilter(CanFilter.Std, (uint)CanAccCode.All, (uint)CanAccMask.All);
      control.StartLine();

      var hello = new CanMessage();
      hello.FrameType = CanMsgFrameType.Data;
      hello.Identifier = 0x100;
      hello.DataLength = 3;
      for (byte i = 0; i < 3; i++) hello[i] = (byte)(i + 1);
      writer.SendMessage(hello);
      Console.WriteLine("sent 100 01 02 03");

      DateTime end = DateTime.Now.AddSeconds(10);
      while (DateTime.Now < end)
      {
        received.WaitOne(100);
        CanMessage m;
        while (reader.ReadMessage(out m))
        {
          if (m.FrameType != CanMsgFrameType.Data || m.Identifier != 0x200) continue;
          string text = "got 200";
          var answer = new CanMessage();
          answer.Identifier = 0x101;
          answer.DataLength = m.DataLength;
          for (int i = 0; i < m.DataLength; i++)
          {
            text += " " + m[i].ToString("X2");
            answer[i] = (byte)(m[i] + 1);
          }
          Console.WriteLine(text);
          writer.SendMessage(answer);
          Thread.Sleep(50);  // it goes out before the channel closes
          Console.WriteLine("sent 101");
          return 0;
        }
      }
      Console.Error.WriteLine("dotnet_talk: no 200h within 10 s");
      return 1;
    }
  }
}
