// The code fragments of the VCI .NET manual (VCI 3, "Handbuch VCI .Net-API", sections
// 4.2.3.1, 4.2.3.2, 4.2.4.1 and 4.3.3.1) as the digest transcribes them, compiled unchanged
// against vcinet2.dll, and a Main that runs them against canemud: "beta" talks at 125 kbit/s (acknowledged by "gamma"),
// "alpha" finds that rate with AutoInitLine, sends with Send, and beta reads with both
// DoMessages; on the LIN bus a [[lin_node]] commander talks and alpha's monitor reads.
//
// One change: the manual's Send declares `messages` and then writes `message[0]` ...
// `message.Length`; those ten `message` are `messages` here (docs/dotnet.md). Everything
// else is the manual's text, its duplicated line and its comments included.
//
//   CANEMU_SOCKET=... MONO_PATH=build/lib mono build/bin/vci_manual_examples.exe
using System;
using System.Collections;
using System.Threading;
using Ixxat.Vci3;
using Ixxat.Vci3.Bal;
using Ixxat.Vci3.Bal.Can;
using Ixxat.Vci3.Bal.Lin;

class CanReceiveSingle
{
  // 4.2.3.1, the first fragment
  public static int Count;

  public static void DoMessages( ICanMessageReader reader )
  {
     CanMessage message;
     while( reader.ReadMessage(out message) )
     {
        // Verarbeitung der Nachricht
        if (Wanted(message)) { Count++; Console.WriteLine("ReadMessage: " + Text(message)); }
     }
  }

  // The frames of Send (not beta's cyclic one, which may still be on its way).
  public static bool Wanted(CanMessage m)
  {
    return m.FrameType == CanMsgFrameType.Data && m.Identifier != 0x7E5;
  }

  public static string Text(CanMessage m)
  {
    string s = string.Format("{0:X3}{1} [{2}]", m.Identifier, m.RemoteTransmissionRequest ? " RTR" : "", m.DataLength);
    for (int i = 0; i < m.DataLength && !m.RemoteTransmissionRequest; i++) s += " " + m[i].ToString("X2");
    return s;
  }
}

class CanReceiveMany
{
  public static int Count;

  // 4.2.3.1, the second fragment
  public static void DoMessages( ICanMessageReader reader )
  {
     CanMessage[] messages = new CanMessage[10];

     int readCount = reader.ReadMessages(messages);
     for( int i = 0; i < readCount; i++ )
     {
        // Verarbeitung der Nachricht
        if (CanReceiveSingle.Wanted(messages[i])) { Count++; Console.WriteLine("ReadMessages: " + CanReceiveSingle.Text(messages[i])); }
     }
  }
}

class CanSend
{
  // 4.2.3.2
  public static bool Send( ICanMessageWriter writer)
  {
     CanMessage[] messages = new CanMessage[3];

     // CAN Nachrichten initialisieren.
     messages[0].Identifier = 0x100;
     messages[0].DataLength = 0;

     messages[1].Identifier = 0x200;
     messages[1].DataLength = 3;
     messages[1].RemoteTransmissionRequest = true;

     messages[2].Identifier = 0x300;
     messages[2].DataLength = 2;
     messages[2].DataLength = 2;
     messages[2][0] = 0x01;
     messages[2][1] = 0xAF;

     return ( messages.Length == writer.SendMessages(messages) );
  }
}

class CanAutoInit
{
  // 4.2.4.1
  public static void AutoInitLine( ICanControl control )
  {
      // Bitrate ermitteln
      int index = control.DetectBaud(10000, CanBitrate.CiaBitRates);

      if (-1 < index)
          {
              CanOperatingModes mode;
              mode = CanOperatingModes.Standard | CanOperatingModes.ErrFrame;
              control.InitLine(mode, CanBitrate.CiaBitRates[index]);
          }
  }
}

class LinReceiveSingle
{
  // 4.3.3.1, the first fragment
  public static int Count;

  public static void DoMessages( ILinMessageReader reader )
  {
    LinMessage message;
    while( reader.ReadMessage(out message) )
     {
       // Verarbeitung der Nachricht
       if (message.MessageType == LinMessageType.Data && Count++ == 0) Console.WriteLine("LIN ReadMessage: " + Text(message));
    }
  }

  public static string Text(LinMessage m)
  {
    string s = string.Format("{0:X2} [{1}]", m.ProtId, m.DataLength);
    for (int i = 0; i < m.DataLength; i++) s += " " + m[i].ToString("X2");
    return s;
  }
}

class LinReceiveMany
{
  public static int Count;

  // 4.3.3.1, the second fragment
  public static void DoMessages( ILinMessageReader reader )
  {
    LinMessage[] messages = new LinMessage[10];
    int readCount = reader.ReadMessages(messages);

  for( int i = 0; i < readCount; i++ )
  {
      // Verarbeitung der Nachricht
      if (messages[i].MessageType == LinMessageType.Data && Count++ == 0) Console.WriteLine("LIN ReadMessages: " + LinReceiveSingle.Text(messages[i]));
  }
  }
}

static class Program
{
  static IVciDevice Find(string name)
  {
    IVciDeviceManager manager = VciServer.GetDeviceManager();
    IVciDeviceList list = manager.GetDeviceList();
    IEnumerator e = list.GetEnumerator();
    while (e.MoveNext())
    {
      IVciDevice d = (IVciDevice)e.Current;
      if (d.Description.Contains("canemu " + name + ")")) return d;
    }
    throw new Exception("no adapter " + name);
  }

  static int Main()
  {
    using (IBalObject gamma = Find("gamma").OpenBusAccessLayer())
    using (IBalObject beta = Find("beta").OpenBusAccessLayer())
    using (IBalObject alpha = Find("alpha").OpenBusAccessLayer())
    {
      // gamma acknowledges at 125 kbit/s; beta sends a cyclic message every 10 ms, so that
      // DetectBaud hears traffic.
      ICanControl gammaControl = (ICanControl)gamma.OpenSocket(0, typeof(ICanControl));
      gammaControl.InitLine(CanOperatingModes.Standard, CanBitrate.Cia125KBit);
      gammaControl.StartLine();
      ICanControl betaControl = (ICanControl)beta.OpenSocket(0, typeof(ICanControl));
      ICanChannel betaChannel = (ICanChannel)beta.OpenSocket(0, typeof(ICanChannel));
      betaChannel.Initialize(64, 16, false);
      ICanMessageReader betaReader = betaChannel.GetMessageReader();
      betaChannel.Activate();
      betaControl.InitLine(CanOperatingModes.Standard, CanBitrate.Cia125KBit);
      betaControl.StartLine();
      ICanScheduler scheduler = (ICanScheduler)beta.OpenSocket(0, typeof(ICanScheduler));
      CanCyclicTXMsg cyclic = new CanCyclicTXMsg();
      cyclic.Identifier = 0x7E5;
      cyclic.DataLength = 1;
      cyclic.CycleTicks = 10;
      scheduler.AddMessage(cyclic);
      scheduler.StartMessage(cyclic);
      scheduler.Resume();

      ICanControl control = (ICanControl)alpha.OpenSocket(0, typeof(ICanControl));
      CanAutoInit.AutoInitLine(control);
      Console.WriteLine("AutoInitLine: " + control.LineStatus.Bitrate);
      scheduler.Suspend();
      ICanChannel channel = (ICanChannel)alpha.OpenSocket(0, typeof(ICanChannel));
      channel.Initialize(64, 16, false);
      ICanMessageWriter writer = channel.GetMessageWriter();
      channel.Activate();
      control.StartLine();
      Thread.Sleep(50);
      CanMessage drop;
      while (betaReader.ReadMessage(out drop)) { }
      Console.WriteLine("Send: " + CanSend.Send(writer));
      for (int i = 0; i < 500 && CanReceiveSingle.Count < 3; i++) { Thread.Sleep(10); CanReceiveSingle.DoMessages(betaReader); }
      Console.WriteLine("Send: " + CanSend.Send(writer));
      for (int i = 0; i < 500 && CanReceiveMany.Count < 3; i++) { Thread.Sleep(10); CanReceiveMany.DoMessages(betaReader); }

      // LIN: alpha's LIN controller (port 1) as a slave at the commander's 19200 bit/s.
      ILinControl lin = (ILinControl)alpha.OpenSocket(1, typeof(ILinControl));
      ILinMonitor monitor = (ILinMonitor)alpha.OpenSocket(1, typeof(ILinMonitor));
      monitor.Initialize(64, false);
      ILinMessageReader linReader = monitor.GetMessageReader();
      monitor.Activate();
      LinInitLine init = new LinInitLine();
      init.OperatingMode = LinOperatingModes.Slave;
      init.Bitrate = LinBitrate.Lin19200Bit;
      lin.InitLine(init);
      lin.StartLine();
      for (int i = 0; i < 500 && LinReceiveSingle.Count == 0; i++) { Thread.Sleep(10); LinReceiveSingle.DoMessages(linReader); }
      for (int i = 0; i < 500 && LinReceiveMany.Count == 0; i++) { Thread.Sleep(10); LinReceiveMany.DoMessages(linReader); }
      return 0;
    }
  }
}
